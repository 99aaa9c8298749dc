"""Document 002 (robot dynamics: RNEA, Lagrange, ABA, friction, contact, identification,
the mobile base), claim by claim: the document's code and formulas transcribed here as it
prints them, set against ours. Each test asserts the value the ledger's row
(youbot_dynamics/studies/ledger_data/doc002.yaml) gives as ours."""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
import sympy as sp

import youbot_dynamics.cli as cli
from youbot_dynamics.dynamics import friction
from youbot_dynamics.dynamics.contact import hunt_crossley_force, newton_impulse, regularised_coulomb
from youbot_dynamics.identification.estimation import ordinary_least_squares
from youbot_dynamics.identification.excitation import FourierTrajectory
from youbot_dynamics.identification.regressor import RegressorLayout, random_samples
from youbot_dynamics.integrate.integrators import DivergenceError, integrate
from youbot_dynamics.studies import planar_base_parameters as planar
from youbot_dynamics.studies.unicycle import Unicycle, simulate_unicycle, unicycle_closed_form, unicycle_rhs

ARM = planar.PlanarArm()  # l1 0.7 m, m1 2 kg, c1 0.3 m, I1 0.05, m2 1.5 kg, c2 0.25 m, I2 0.03


# --------------------------------------------------------------------------------------
# Newton-Euler: the document's NewtonEulerDynamics.compute_torques, as printed
# --------------------------------------------------------------------------------------
def document_compute_torques(links, q, qd, qdd):
    """The document's code line by line (gravity [0, 0, -9.81]; F_ext unused there too)."""
    n = len(links)
    omega, omega_d, v_d = np.zeros((n + 1, 3)), np.zeros((n + 1, 3)), np.zeros((n + 1, 3))
    v_d[0] = -np.array([0, 0, -9.81])
    for i in range(n):
        R, r = links[i]["parent_transform"][:3, :3], links[i]["parent_transform"][:3, 3]
        z = links[i]["joint_axis"]
        omega[i + 1] = R.T @ omega[i]
        omega_d[i + 1] = R.T @ omega_d[i]
        omega[i + 1] += qd[i] * z
        omega_d[i + 1] += qdd[i] * z + np.cross(omega[i], qd[i] * z)
        v_d[i + 1] = R.T @ (v_d[i] + np.cross(omega_d[i], r) + np.cross(omega[i], np.cross(omega[i], r)))
    n_torque, tau = np.zeros((n + 1, 3)), np.zeros(n)
    for i in range(n - 1, -1, -1):
        link = links[i]
        inertia = link["inertia"]
        n_torque[i] = inertia @ omega_d[i + 1] + np.cross(omega[i + 1], inertia @ omega[i + 1])
        tau[i] = n_torque[i].T @ link["joint_axis"] + qd[i] * link.get("fv", 0.0) \
            + np.sign(qd[i]) * link.get("fc", 0.0)
    return tau


def document_links(arm: planar.PlanarArm):
    """The planar arm in the document's link dictionaries (joint axis y, fixed transforms)."""
    def transform(x):
        t = np.eye(4)
        t[0, 3] = x
        return t
    return [{"mass": m, "inertia": np.eye(3) * i, "com": np.array([c, 0.0, 0.0]),
             "joint_axis": np.array([0.0, 1.0, 0.0]), "parent_transform": transform(x)}
            for m, i, c, x in ((arm.m1, arm.I1, arm.c1, 0.0), (arm.m2, arm.I2, arm.c2, arm.l1))]


def test_document_rnea_code_never_uses_q_nor_the_child_links():
    """The printed code reads q nowhere (the fixed parent_transform is never turned by the
    joint) and sums no child force into its parent (tau_i = n_i . z of link i alone, with
    f_i computed and dropped): its torques are I1 a1 and I2 (a1 + a2), with no gravity.
    Ours (Pinocchio's RNEA) holds the level arm at rest against gravity."""
    robot = planar.robot(ARM)
    data = robot.model.createData()
    links = document_links(ARM)
    rest = np.zeros(2)
    ours = pin.rnea(robot.model, data, rest, rest, rest)
    # measured -19.865 and -3.679 N m: -g (m1 c1 + m2 (l1 + c2)) and -g m2 c2
    np.testing.assert_allclose(ours, [-9.81 * (ARM.m1 * ARM.c1 + ARM.m2 * (ARM.l1 + ARM.c2)),
                                      -9.81 * ARM.m2 * ARM.c2], rtol=1e-12)
    assert np.array_equal(document_compute_torques(links, rest, rest, rest), [0.0, 0.0])
    rng = np.random.default_rng(2)
    for _ in range(5):
        q, v, a = rng.uniform(-2, 2, (3, 2))
        printed = document_compute_torques(links, q, v, a)
        np.testing.assert_array_equal(printed, document_compute_torques(links, -q, v, a))
        np.testing.assert_allclose(printed, [ARM.I1 * a[0], ARM.I2 * (a[0] + a[1])], rtol=1e-14, atol=1e-15)
        assert np.abs(printed - pin.rnea(robot.model, data, q, v, a)).max() > 1.0


def printed_recursion(arm: planar.PlanarArm, q, qd, qdd, transport: bool):
    """The printed RNEA on the planar arm, frames at the joints turned by q (R_i = Ry(q_i)):
    the forward phase of the equations (the code's, with R turned), then the printed backward
    phase F_i = R F_{i+1} + [f_i; n_i + c_i x f_i], tau_i = F_i . z (moment part), with
    ``transport`` adding the moment the printed phase leaves out, r_{i+1} x (R f_{i+1})."""
    z, gravity_up = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 9.81])
    offsets = [np.zeros(3), np.array([arm.l1, 0.0, 0.0])]
    coms = [np.array([arm.c1, 0.0, arm.d1]), np.array([arm.c2, 0.0, arm.d2])]
    masses, inertias = (arm.m1, arm.m2), (np.eye(3) * arm.I1, np.eye(3) * arm.I2)
    turns = [pin.utils.rotate("y", angle) for angle in q]
    omega, omega_d, v_d = [np.zeros(3)], [np.zeros(3)], [gravity_up]
    for i in range(2):
        R, r = turns[i], offsets[i]
        v_d.append(R.T @ (v_d[i] + np.cross(omega_d[i], r) + np.cross(omega[i], np.cross(omega[i], r))))
        omega.append(R.T @ omega[i] + qd[i] * z)
        omega_d.append(R.T @ omega_d[i] + qdd[i] * z + np.cross(R.T @ omega[i], qd[i] * z))
    force, moment, tau = np.zeros(3), np.zeros(3), np.zeros(2)
    for i in (1, 0):
        w, w_d, c = omega[i + 1], omega_d[i + 1], coms[i]
        f = masses[i] * (v_d[i + 1] + np.cross(w_d, c) + np.cross(w, np.cross(w, c)))
        n = inertias[i] @ w_d + np.cross(w, inertias[i] @ w)
        R = turns[i + 1] if i + 1 < 2 else np.eye(3)
        carried = R @ moment + (np.cross(offsets[i + 1], R @ force) if transport and i + 1 < 2 else 0.0)
        force, moment = R @ force + f, carried + n + np.cross(c, f)
        tau[i] = moment @ z
    return tau


def test_printed_backward_phase_misses_the_childs_moment_arm():
    """The printed backward phase carries the child's wrench by the rotation alone: with the
    moment r_{i+1} x (R f_{i+1}) added it is Pinocchio's RNEA to 1e-12 N m at random states
    (COMs off the link axes); as printed, the level arm at rest gets tau1 = -g (m1 c1 + m2 c2)
    = -9.565 N m where Pinocchio (and the completed recursion) hold it with -19.865 N m: the
    missing -g m2 l1 = -10.30 N m."""
    arm = planar.PlanarArm(d1=0.04, d2=-0.03)
    robot = planar.robot(arm)
    data = robot.model.createData()
    rng = np.random.default_rng(9)
    for _ in range(10):
        q, v, a = rng.uniform(-2, 2, (3, 2))
        np.testing.assert_allclose(printed_recursion(arm, q, v, a, transport=True),
                                   pin.rnea(robot.model, data, q, v, a), rtol=0, atol=1e-12)
    rest = np.zeros(2)
    printed = printed_recursion(ARM, rest, rest, rest, transport=False)
    np.testing.assert_allclose(printed, [-9.81 * (ARM.m1 * ARM.c1 + ARM.m2 * ARM.c2), -9.81 * ARM.m2 * ARM.c2],
                               rtol=1e-12)
    assert math.isclose(printed[0], -9.565, rel_tol=1e-3)
    completed = printed_recursion(ARM, rest, rest, rest, transport=True)
    assert math.isclose(completed[0] - printed[0], -9.81 * ARM.m2 * ARM.l1, rel_tol=1e-12)


# --------------------------------------------------------------------------------------
# Lagrange
# --------------------------------------------------------------------------------------
def test_lagrange_form_by_sympy_equals_pinocchio_rnea():
    """M(q) q'' + C(q, q') q' + G(q) = tau from L = T - U (sympy) against Pinocchio's RNEA on
    the arm with its centres of mass off the link axes: equal to 1e-12 N m (measured 3.6e-15)."""
    arm = planar.PlanarArm(d1=0.04, d2=-0.03)
    robot = planar.robot(arm)
    data = robot.model.createData()
    tau, _ = planar.symbolic_torques()
    values = dict(zip(planar.SYMBOLS, [arm.l1, arm.m1, arm.c1, arm.d1, arm.I1, arm.m2, arm.c2, arm.d2,
                                       arm.I2, arm.g]))
    numeric = sp.lambdify([*planar.Q, *planar.V, *planar.A], tau.subs(values), "numpy")
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(10):
        q, v, a = rng.uniform(-2, 2, (3, 2))
        worst = max(worst, np.abs(np.ravel(numeric(*q, *v, *a)) - pin.rnea(robot.model, data, q, v, a)).max())
    assert worst < 1e-12


def test_our_lagrange_m11_is_the_kinetic_energy_the_printed_code_drops():
    """The printed symbolic_dynamics sets T_total = 0 and never adds to it: its tau is
    dU/dq, G(q) alone (M = 0). Ours has M11 = ZZ1R + ZZ2 + 2 l1 MX2 = 1.61375 kg m^2 at q2 = 0."""
    _, mass = planar.symbolic_torques()
    values = dict(zip(planar.SYMBOLS, [ARM.l1, ARM.m1, ARM.c1, ARM.d1, ARM.I1, ARM.m2, ARM.c2, ARM.d2,
                                       ARM.I2, ARM.g]))
    m11 = float(mass[0, 0].subs(values).subs(planar.Q[1], 0.0))
    assert math.isclose(m11, 0.965 + 0.12375 + 2 * 0.7 * 0.375, rel_tol=1e-12)  # 1.61375


# --------------------------------------------------------------------------------------
# Friction
# --------------------------------------------------------------------------------------
def document_viscous_coulomb(qd, fv, fc, fs=0.0, vs=0.01, sigma=100.0):
    """FrictionModel.viscous_coulomb as printed."""
    return fv * qd + fc * np.tanh(sigma * qd) + (fs - fc) * np.exp(-(qd / vs) ** 2)


def document_lugre(z, qd, sigma0, sigma1, sigma2, fc):
    """FrictionModel.luGre as printed."""
    z_dot = qd - sigma0 * abs(qd) / fc * z
    return sigma0 * z + sigma1 * z_dot + sigma2 * qd, z_dot


def test_viscous_coulomb_part_is_ours_with_the_default_scale():
    """sigma = 100 is our default regularisation v_s = 1 / sigma = 0.01 rad/s: away from rest
    (|qd| >= 0.1 rad/s, where exp(-(qd / vs)^2) < 4e-44) the document's law is our coulomb law
    F_c tanh(v / v_s) + b v to 1e-15."""
    assert friction.DEFAULT_VELOCITY_SCALE == 1.0 / 100.0
    qd = np.concatenate([np.linspace(-3, -0.1, 30), np.linspace(0.1, 3, 30)])
    ours = friction.coulomb(qd, 0.8, friction.DEFAULT_VELOCITY_SCALE) + friction.viscous(qd, 0.2)
    np.testing.assert_allclose(document_viscous_coulomb(qd, 0.2, 0.8, fs=0.8), ours, rtol=0, atol=1e-15)


def test_document_stribeck_term_is_even_and_ours_is_odd():
    """The printed Stribeck term (fs - fc) exp(-(qd / vs)^2) has no sign(qd): at rest the
    default fs = 0 gives -fc (here -1 N m, friction with no motion), and with fs = 1.5 it
    pushes along a negative motion. Ours multiplies the Stribeck curve by tanh(v / v_s): odd,
    0 at rest. At qd = -0.005 rad/s (fv 0.1, fc 1, fs 1.5): document -0.0732, ours -0.6426 N m."""
    assert document_viscous_coulomb(0.0, 0.1, 1.0) == -1.0
    assert friction.stribeck(0.0, 1.0, 1.5, 0.01, 0.01) == 0.0
    printed = document_viscous_coulomb(-0.005, 0.1, 1.0, fs=1.5)
    ours = friction.stribeck(-0.005, 1.0, 1.5, 0.01, 0.01) + friction.viscous(-0.005, 0.1)
    assert math.isclose(printed, -0.0732, abs_tol=5e-5) and math.isclose(ours, -0.6426, abs_tol=5e-5)
    assert math.isclose(ours, -(friction.stribeck(0.005, 1.0, 1.5, 0.01, 0.01) + friction.viscous(0.005, 0.1)),
                        rel_tol=1e-15)
    assert not math.isclose(printed, -document_viscous_coulomb(0.005, 0.1, 1.0, fs=1.5), rel_tol=0.5)


def test_lugre_is_ours_with_the_static_level_at_coulomb():
    """The document's LuGre (g(v) = fc) is our law with F_s = F_c, to 1e-15 (measured 0)."""
    rng = np.random.default_rng(4)
    z, qd = rng.normal(0, 1e-3, 50), rng.normal(0, 1, 50)
    printed, rate = document_lugre(z, qd, 1e4, 30.0, 0.4, 2.0)
    np.testing.assert_allclose(friction.lugre(qd, z, 1e4, 30.0, 0.4, 2.0, 2.0, 0.05), printed, rtol=1e-15,
                               atol=1e-15)
    np.testing.assert_allclose(friction.lugre_bristle_rate(qd, z, 1e4, 2.0, 2.0, 0.05), rate, rtol=1e-15,
                               atol=1e-15)


# --------------------------------------------------------------------------------------
# Contact
# --------------------------------------------------------------------------------------
def test_document_contact_force_pulls_where_ours_does_not():
    """ContactModel(k = 1e6, b = 1e3): fn = k d + b d'. At d = 1e-4 m separating at 0.5 m/s
    it is -400 N (pulls); at first touch (d = 0+, d' = 1 m/s) it jumps to 1000 N. Ours, Hunt
    and Crossley k d^n (1 + chi d'), clipped at 0 (n = 1, chi = 1 s/m): 50 N and 0 N there,
    never negative for any chi; equal to the document's without motion (d' = 0: 100 N both)."""
    k, b = 1e6, 1e3     # the document's k d + b d': 1e6 * 1e-4 + 1e3 * -0.5 = -400 N, 0 + 1e3 * 1 = 1000 N
    assert math.isclose(hunt_crossley_force(1e-4, -0.5, k, 1.0, 1.0), 50.0, rel_tol=1e-12)
    assert hunt_crossley_force(1e-12, 1.0, k, 1.0, 1.0) < 1e-5
    assert min(hunt_crossley_force(1e-4, rate, k, 1.0, chi) for rate in np.linspace(-5, 0, 11)
               for chi in (0.1, 1.0, 10.0)) == 0.0
    assert hunt_crossley_force(1e-4, 0.0, k, 1.0, 1.0) == 100.0     # k d, the document's at d' = 0


def test_contact_friction_is_ours_away_from_the_regularisation():
    """ft = -mu |fn| u / |u| (mu 0.5) against ours -mu fn u / sqrt(|u|^2 + v_s^2), v_s 1e-3
    m/s: relative gap v_s^2 / (2 |u|^2) = 5e-5 at 0.1 m/s."""
    u = np.array([0.06, -0.08, 0.0])  # 0.1 m/s
    printed = -0.5 * 200.0 * u / np.linalg.norm(u)
    ours = regularised_coulomb(u, 200.0, 0.5, 1e-3)
    assert math.isclose(np.linalg.norm(ours - printed) / np.linalg.norm(printed), 5e-5, rel_tol=1e-3)


def document_impulse(relative_velocity, normal, m1, m2, mu=0.5, restitution=0.3):
    """ContactModel.compute_impulse as printed (its garbled constants read 0, 1, 1e-6)."""
    vn = np.dot(relative_velocity, normal)
    if vn >= 0:
        return np.zeros(3)
    w = 1 / m1 + 1 / m2
    jn = -(1 + restitution) * vn / w
    impulse = jn * normal
    vt = relative_velocity - vn * normal
    if np.linalg.norm(vt) > 1e-6:
        jt = min(mu * jn, np.linalg.norm(vt) / w)
        impulse -= jt * vt / np.linalg.norm(vt)
    return impulse


@pytest.mark.parametrize("tangential", [0.2, 5.0], ids=["sticking", "sliding"])
def test_impulse_is_ours(tangential):
    """Newton's law e = 0.3 with the Coulomb cone, two point masses (2 and 3 kg): the
    document's impulse equals ours to 1e-14 N s, sticking and sliding."""
    normal = np.array([0.0, 0.0, 1.0])
    velocity = np.array([tangential, 0.0, -1.0])
    ours, _ = newton_impulse(np.eye(3) * (1 / 2 + 1 / 3), velocity, normal, 0.3, 0.5)
    np.testing.assert_allclose(document_impulse(velocity, normal, 2.0, 3.0), ours, rtol=0, atol=1e-14)


# --------------------------------------------------------------------------------------
# Identification
# --------------------------------------------------------------------------------------
def test_excitation_series_is_ours():
    """q_j(t) = sum_k a_k / (w_f k) sin(w_f k t) - b_k / (w_f k) cos(w_f k t), five
    harmonics, w_f = 2 pi / 20 s, 100 Hz: our FourierTrajectory (q0 = 0) to 1e-15 rad."""
    rng = np.random.default_rng(1)
    a, b = rng.uniform(-1, 1, (2, 1, 5))
    t = np.linspace(0, 20, 20 * 100)
    omega_f = 2 * np.pi / 20
    printed = sum(a[0, k - 1] / (omega_f * k) * np.sin(omega_f * k * t)
                  - b[0, k - 1] / (omega_f * k) * np.cos(omega_f * k * t) for k in range(1, 6))
    q, _, _ = FourierTrajectory(("j",), 20.0, np.zeros(1), a, b).evaluate(t)
    np.testing.assert_allclose(q[:, 0], printed, rtol=0, atol=1e-14)
    # `excite`'s defaults: 5 harmonics and 100 Hz as the document, a 10 s period against its 20 s
    args = cli.build_parser(("youbot_dynamics.cli.identify_commands",)).parse_args(["excite"])
    assert (args.harmonics, args.rate, args.period) == (5, 100.0, 10.0)


def test_least_squares_is_ours_and_the_condition_is_of_y():
    """Theta = (Y^T Y)^-1 Y^T tau (the code's W = I): our OLS to 1e-12. Its covariance divides
    the residual's variance about its mean by N (np.var), ours its mean square by N - p
    (unbiased): ours is 1.0551 times the document's here (N / (N - p) = 1.0526 at N = 200,
    p = 10); its condition number is of Y^T Y, ours of Y: the square root of it."""
    rng = np.random.default_rng(6)
    y = rng.normal(size=(200, 10)) * np.logspace(0, 1, 10)
    tau = y @ rng.normal(size=10) + rng.normal(0, 0.1, 200)
    theta = np.linalg.pinv(y.T @ y) @ y.T @ tau
    residuals = tau - y @ theta
    covariance = np.var(residuals) * np.linalg.inv(y.T @ y)
    ours = ordinary_least_squares(y, tau, 1)
    np.testing.assert_allclose(ours.values, theta, rtol=0, atol=1e-12)
    n, p = y.shape
    factor = n / (n - p) * np.mean(residuals ** 2) / np.var(residuals)     # 1.0551446 here
    np.testing.assert_allclose(ours.covariance, covariance * factor, rtol=1e-9)
    assert factor == pytest.approx(1.0551, abs=1e-4)     # the figure the docstring and ledger give
    assert math.isclose(ours.condition ** 2, np.linalg.cond(y.T @ y), rel_tol=1e-9)


def test_planar_base_parameters_three_ways():
    """The 2-DOF planar example (studies/planar_base_parameters.py): 6 base parameters with
    gravity in the plane, 4 without (not the document's 6 + 6 + 5 n = 22); QR's K spans the
    sympy groups (residual < 1e-12, measured 6.7e-16); the torques hold the masses, centres of
    mass and inertias only through the groups; the document's list is M11 - I2, M22 (= ZZ2)
    and (M12 - ZZ2) / l1."""
    result = planar.run()
    assert (result.vertical.count, result.horizontal.count) == (6, 4)
    assert max(result.row_space_gap.values()) < 1e-12
    assert result.grouped_free
    assert result.document_minus_ours == ("-I2", "0", "0")
    assert math.isclose(result.values["ZZ2"], 0.12375, rel_tol=1e-12)


# --------------------------------------------------------------------------------------
# The mobile base
# --------------------------------------------------------------------------------------
def document_unicycle(state, u, m=10.0, inertia=0.5, r=0.05, wheel_base=0.3, b=1.0, beta=0.5):
    """UnicycleDynamics.dynamics as printed."""
    _, _, theta, v, omega = state
    tau_l, tau_r = u
    force = (tau_l + tau_r) / r
    torque = (tau_r - tau_l) * (wheel_base / (2 * r))
    return np.array([v * np.cos(theta), v * np.sin(theta), omega, (force - b * v) / m,
                     (torque - beta * omega) / inertia])


def test_unicycle_dynamics_are_ours_with_the_documents_defaults():
    """Our Unicycle() is the document's (m 10, I 0.5, r 0.05, L 0.3, b 1, beta 0.5): the
    right-hand sides agree to 1e-15 at random states and torques."""
    model = Unicycle()
    rng = np.random.default_rng(8)
    for state, (tau_l, tau_r) in zip(rng.normal(size=(20, 5)), rng.normal(size=(20, 2))):
        np.testing.assert_allclose(unicycle_rhs(0.0, state, model, lambda t: (tau_r, tau_l)),
                                   document_unicycle(state, (tau_l, tau_r)), rtol=1e-15, atol=1e-15)


def test_rk4_at_one_millisecond_over_five_seconds():
    """simulate_robot's RK4, dt = 1 ms, T = 5 s, on the document's unicycle driving straight
    (0.4 N m each wheel): ours within 1e-10 of the closed form (measured 1.7e-12)."""
    model = Unicycle()
    solution = simulate_unicycle(model, 0.4, 0.4, 5.0, "rk4", dt=1e-3, n_out=51)
    closed = np.array([unicycle_closed_form(model, 0.4, 0.4, np.zeros(5), t) for t in solution.t])
    assert np.abs(solution.x - closed).max() < 1e-10


# --------------------------------------------------------------------------------------
# The pitfalls ("Pièges et bonnes pratiques")
# --------------------------------------------------------------------------------------
def spring(stiffness: float, mass: float = 1.0):
    """x'' = -(k / m) x as x' = (position, velocity)."""
    return lambda t, x: np.array([x[1], -stiffness / mass * x[0]])


def test_mass_matrix_stays_positive_definite_at_the_kinematic_singularity():
    """'M(q) becomes ill-conditioned near kinematic singularities; its inverse may explode':
    on the planar arm M is worst conditioned stretched out (q2 = 0, where the Jacobian loses
    rank): condition number 57.8 against 10.2 at q2 = pi/2, but its determinant ZZ1R ZZ2 -
    (l1 MX2 cos q2)^2 stays at or above 0.0505 kg^2 m^4 > 0 for every q2: M^-1 is bounded."""
    _, mass = planar.symbolic_torques()
    values = dict(zip(planar.SYMBOLS, [ARM.l1, ARM.m1, ARM.c1, ARM.d1, ARM.I1, ARM.m2, ARM.c2, ARM.d2,
                                       ARM.I2, ARM.g]))
    numeric = sp.lambdify(planar.Q[1], mass.subs(values), "numpy")
    q2 = np.linspace(-np.pi, np.pi, 721)
    matrices = np.array([numeric(angle) for angle in q2], dtype=float)
    conditions = np.linalg.cond(matrices)
    assert math.isclose(conditions[360], 57.8, rel_tol=1e-3) and math.isclose(conditions[540], 10.2, rel_tol=1e-2)
    assert conditions.argmax() == 360  # q2 = 0: stretched out (folded, q2 = pi: 7.2)
    determinants = np.linalg.det(matrices)
    assert math.isclose(determinants.min(), 0.965 * 0.12375 - (0.7 * 0.375) ** 2, rel_tol=1e-9)  # 0.0505


def test_contact_stiffness_limit_of_rk4_at_one_millisecond():
    """'k > 1e7 -> unstable integration': RK4 at dt = 1 ms on a 1 kg contact spring is stable
    for h sqrt(k / m) < 2.785 (its real-axis stability limit), k < 7.76e6 N/m. Ours: k = 1e6
    stays within its 1e-3 m amplitude over 1 s; k = 1e7 grows past 1e10 m (measured: it
    overflows, a DivergenceError at t = 0.935 s)."""
    t = np.linspace(0.0, 1.0, 11)
    soft = integrate(spring(1e6), [1e-3, 0.0], t, "rk4", dt=1e-3)
    assert np.abs(soft.x[:, 0]).max() <= 1e-3 * (1 + 1e-9)
    with np.errstate(over="ignore", invalid="ignore"):
        try:
            stiff = np.abs(integrate(spring(1e7), [1e-3, 0.0], t, "rk4", dt=1e-3).x[-1, 0])
        except DivergenceError:
            stiff = math.inf
    assert stiff > 1e10


def test_semi_implicit_euler_keeps_the_energy_explicit_euler_does_not():
    """'Semi-implicit Euler (symplectic) more stable for mechanical systems': on the spring
    k = 1e4 N/m, m = 1 kg at dt = 1 ms over 2 s, explicit Euler's energy grows by
    (1 + h^2 k / m)^N = 1.01^2000 = 4.4e8; symplectic Euler's stays within its modified
    energy's bound (h w / 2) / (1 - h w / 2) = 5.263 % (h w = 0.1; measured 5.2630 %)."""
    t = np.linspace(0.0, 2.0, 201)

    def energy(x):
        return 0.5 * x[:, 1] ** 2 + 0.5 * 1e4 * x[:, 0] ** 2
    explicit = integrate(spring(1e4), [0.01, 0.0], t, "euler", dt=1e-3).x
    symplectic = integrate(spring(1e4), [0.01, 0.0], t, "symplectic_euler", dt=1e-3, n_positions=1).x
    growth = energy(explicit)[-1] / energy(explicit)[0]
    assert math.isclose(growth, (1 + 1e-6 * 1e4) ** 2000, rel_tol=1e-6)
    assert np.abs(energy(symplectic) / energy(symplectic)[0] - 1).max() < 0.0527


def test_full_inertial_parameters_are_not_identifiable():
    """'Identifying every individual parameter is under-determined': the planar arm's
    stacked regressor has rank 6 of its 20 inertial columns, so Y^T Y is singular (the 7th
    singular value is 9.6e-17 of the first); the 6 base columns are well posed (condition
    number 13.3, bound 1e3)."""
    layout = RegressorLayout(planar.robot(ARM), friction_terms=())
    q, v, a = random_samples(layout.robot, 200, np.random.default_rng(0))
    stacked = layout.stacked(q, v, a)
    assert stacked.shape[1] == 20 and np.linalg.matrix_rank(stacked) == 6
    base = planar.base_parameters(layout)
    assert np.linalg.cond(base.columns(stacked)) < 1e3
