"""Joint friction laws and JointFriction: closed-form limits, symmetry, bounds, LuGre's steady
state reached by integration, the URDF defaults, and the errors of a bad friction spec."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from youbot_dynamics.dynamics import friction as fr
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import load_robot

URDF = Path(__file__).resolve().parents[2] / "urdf" / "youbot.urdf"
EXTREMES = np.array([0.0, 1e-12, -1e-12, 1e3, -1e3])
LUGRE = {"law": "lugre", "sigma0": 2e3, "sigma1": 5.0, "sigma2": 0.2, "coulomb": 0.5,
         "static": 0.9, "stribeck_velocity": 0.05}
STRIBECK = {"law": "stribeck", "coulomb": 0.4, "static": 0.7, "stribeck_velocity": 0.1,
            "damping": 0.3, "velocity_scale": 1e-3}


@pytest.fixture(scope="module")
def youbot():
    return load_robot(URDF)


@pytest.fixture(scope="module")
def mixed(youbot):
    """Every law on some joint: LuGre on two, Stribeck on one, viscous on one."""
    return JointFriction.from_spec(youbot, {
        "arm_joint_2": LUGRE, "arm_joint_4": {**LUGRE, "sigma0": 500.0, "static": 0.6},
        "arm_joint_3": STRIBECK, "gripper_finger_joint_l": {"law": "viscous", "damping": 2.0}})


def test_coulomb_is_odd_and_bounded():
    v = np.concatenate([EXTREMES, np.random.default_rng(0).normal(0, 0.05, 200)])
    force = fr.coulomb(v, 0.5, 0.01)
    np.testing.assert_array_equal(force, -fr.coulomb(-v, 0.5, 0.01))
    assert np.all(np.abs(force) <= 0.5) and np.all(force * v >= 0)
    assert fr.coulomb(1e3, 0.5, 0.01) == 0.5 and fr.coulomb(0.0, 0.5, 0.01) == 0.0
    # slope at v = 0 is F_c / v_s: smooth, no jump
    assert fr.coulomb(1e-9, 0.5, 0.01) / 1e-9 == pytest.approx(50.0, rel=1e-12)


def test_stribeck_curve_limits():
    assert fr.stribeck_curve(0.0, 0.4, 0.7, 0.1) == 0.7  # static (break-away) level at rest
    assert fr.stribeck_curve(0.1, 0.4, 0.7, 0.1) == pytest.approx(0.4 + 0.3 / np.e, rel=1e-15)
    assert fr.stribeck_curve(10.0, 0.4, 0.7, 0.1) == pytest.approx(0.4, rel=1e-15)  # Coulomb level
    v = np.linspace(-2, 2, 101)
    force = fr.stribeck(v, 0.4, 0.7, 0.1, 1e-3)
    np.testing.assert_array_equal(force, -fr.stribeck(-v, 0.4, 0.7, 0.1, 1e-3))
    assert np.all(np.abs(force) <= 0.7)


def test_urdf_defaults(youbot):
    """Law coulomb with b = URDF damping and F_c = URDF friction on every joint."""
    friction = JointFriction.from_urdf(youbot, velocity_scale=0.02)
    assert friction.laws == ("coulomb",) * youbot.nv and friction.n_states == 0
    for v in (1e3, -1e3):  # tanh saturates to +-1 in double precision
        np.testing.assert_allclose(friction.torque(np.full(youbot.nv, v)),
                                   youbot.damping * v + youbot.friction * np.sign(v), rtol=1e-15)
    np.testing.assert_array_equal(friction.torque(np.zeros(youbot.nv)), 0.0)
    h = 1e-8  # slope at rest: b + F_c / v_s
    np.testing.assert_allclose(friction.torque(np.full(youbot.nv, h)) / h,
                               youbot.damping + youbot.friction / 0.02, rtol=1e-9)
    assert friction.damping.flags.writeable is False


def test_mixed_laws_assemble_per_joint(youbot, mixed):
    """Each joint's torque is its own law with its own parameters."""
    assert mixed.state_names == ("z[arm_joint_2]", "z[arm_joint_4]")
    assert mixed.lugre_joints == ("arm_joint_2", "arm_joint_4")
    rng = np.random.default_rng(1)
    v, z = rng.normal(0, 0.3, youbot.nv), rng.normal(0, 1e-4, 2)
    tau, dz = mixed.torque(v, z), mixed.state_derivative(v, z)
    i2, i3, i4, finger = (youbot.joint_index(n) for n in
                          ("arm_joint_2", "arm_joint_3", "arm_joint_4", "gripper_finger_joint_l"))
    law = {k: val for k, val in LUGRE.items() if k != "law"}
    assert tau[i2] == fr.lugre(v[i2], z[0], **_lugre_args(law))
    assert tau[i4] == fr.lugre(v[i4], z[1], **_lugre_args({**law, "sigma0": 500.0, "static": 0.6}))
    assert dz[0] == fr.lugre_bristle_rate(v[i2], z[0], 2e3, 0.5, 0.9, 0.05)
    assert tau[i3] == pytest.approx(fr.stribeck(v[i3], 0.4, 0.7, 0.1, 1e-3) + 0.3 * v[i3], rel=1e-15)
    assert tau[finger] == 2.0 * v[finger]
    i1 = youbot.joint_index("arm_joint_1")
    assert tau[i1] == pytest.approx(1.0 * v[i1] + fr.coulomb(v[i1], 0.5, fr.DEFAULT_VELOCITY_SCALE), rel=1e-15)


def _lugre_args(p):
    return {"sigma0": p["sigma0"], "sigma1": p["sigma1"], "sigma2": p["sigma2"],
            "coulomb_level": p["coulomb"], "static": p["static"], "stribeck_velocity": p["stribeck_velocity"]}


@pytest.mark.parametrize("velocity", [0.01, 0.05, 0.3, -0.02, -1.0])
def test_lugre_settles_to_stribeck_steady_state(youbot, mixed, velocity):
    """At constant v the bristle state settles and F -> g(v) sign(v) + sigma2 v."""
    v = np.zeros(youbot.nv)
    v[[youbot.joint_index("arm_joint_2"), youbot.joint_index("arm_joint_4")]] = velocity
    solution = solve_ivp(lambda t, z: mixed.state_derivative(v, z), (0.0, 2.0), np.zeros(2),
                         method="Radau", rtol=1e-10, atol=1e-14)
    z_end = solution.y[:, -1]
    force = mixed.torque(v, z_end)[[youbot.joint_index("arm_joint_2"), youbot.joint_index("arm_joint_4")]]
    g = fr.stribeck_curve(velocity, 0.5, np.array([0.9, 0.6]), 0.05)
    np.testing.assert_allclose(force, g * np.sign(velocity) + 0.2 * velocity, rtol=1e-7)
    np.testing.assert_allclose(z_end, mixed.steady_state_bristles(v), rtol=1e-7)


def test_finite_and_bounded_at_extreme_velocities(youbot, mixed):
    for value in EXTREMES:
        v = np.full(youbot.nv, value)
        for z in (mixed.steady_state_bristles(v), np.full(2, 1e-3)):
            tau, dz = mixed.torque(v, z), mixed.state_derivative(v, z)
            assert np.all(np.isfinite(tau)) and np.all(np.isfinite(dz))
            # viscous part plus a bounded part: |F - b v| <= max(F_s, F_c) + sigma0 |z| + sigma1 |dz|
            bound = 1.0 + 2e3 * np.abs(z).max() + 5.0 * np.abs(dz).max() + 1e-9
            viscous_part = (mixed.damping + 0.2 * _is_lugre(mixed)) * v
            assert np.all(np.abs(tau - viscous_part) <= bound)


def _is_lugre(friction):
    return np.array([law == "lugre" for law in friction.laws], dtype=float)


@pytest.mark.parametrize("spec, words", [
    ({"arm_joint_9": {"law": "viscous", "damping": 1}}, ["arm_joint_9", "unknown joint"]),
    ({"arm_joint_1": {"law": "dahl"}}, ["arm_joint_1", "dahl", "law"]),
    ({"arm_joint_1": {"damping": 1}}, ["arm_joint_1", "'law'"]),
    ({"arm_joint_1": {**LUGRE, "sigma1": None}}, ["arm_joint_1", "sigma1"]),
    ({"arm_joint_1": {k: v for k, v in LUGRE.items() if k != "sigma0"}}, ["arm_joint_1", "sigma0"]),
    ({"arm_joint_2": {"law": "viscous", "damping": 1, "stiction": 3}}, ["arm_joint_2", "stiction"]),
    ({"arm_joint_3": {"law": "coulomb", "coulomb": -1, "damping": 0}}, ["arm_joint_3", "coulomb", ">= 0"]),
    ({"arm_joint_3": {**STRIBECK, "stribeck_velocity": 0}}, ["arm_joint_3", "stribeck_velocity", "> 0"]),
    ({"arm_joint_5": {**LUGRE, "coulomb": 0.0}}, ["arm_joint_5", "coulomb"]),
])
def test_bad_spec_names_joint_and_key(youbot, spec, words):
    with pytest.raises(UserInputError) as error:
        JointFriction.from_spec(youbot, spec, where="scene.yaml: friction")
    assert all(word in str(error.value) for word in [*words, "scene.yaml: friction"])


def test_wrong_bristle_state_is_an_error(youbot, mixed):
    with pytest.raises(UserInputError, match="2 LuGre bristle states"):
        mixed.torque(np.zeros(youbot.nv))
    with pytest.raises(UserInputError, match="2 LuGre bristle states"):
        mixed.state_derivative(np.zeros(youbot.nv), np.zeros(3))


def test_batch_rows_and_in_place_forms_equal_the_single_torque(youbot, mixed):
    """torque of a batch (N, n) row by row, add_torque with either sign, and the laws in
    numpy joint by joint: the compiled loop evaluates the same formulas (measured equal; the
    bound allows one rounding of libm's tanh/exp against numpy's)."""
    rng = np.random.default_rng(11)
    v, z = rng.normal(0.0, 0.5, (6, youbot.nv)), rng.normal(0.0, 1e-3, (6, 2))
    rows = np.array([mixed.torque(v[k], z[k]) for k in range(6)])
    np.testing.assert_array_equal(mixed.torque(v, z), rows)
    tau = rng.normal(size=youbot.nv)
    for sign in (1.0, -1.0):
        out = tau.copy()
        mixed.add_torque(out, v[0], z[0], sign)
        np.testing.assert_allclose(out, tau + sign * rows[0], rtol=1e-15, atol=1e-15)
    lugre = [youbot.joint_index("arm_joint_2"), youbot.joint_index("arm_joint_4")]
    i3 = youbot.joint_index("arm_joint_3")
    assert rows[0, lugre[0]] == pytest.approx(fr.lugre(v[0, lugre[0]], z[0, 0], 2e3, 5.0, 0.2, 0.5, 0.9, 0.05),
                                              rel=1e-15)
    assert rows[0, i3] == pytest.approx(0.3 * v[0, i3] + fr.stribeck(v[0, i3], 0.4, 0.7, 0.1, 1e-3), rel=1e-15)


def test_wrong_velocity_size_is_refused_before_the_compiled_loop(youbot, mixed):
    """The compiled loop does not check bounds: a wrong size must stop in Python."""
    z = np.zeros(2)
    for v, out in ((np.zeros(youbot.nv - 1), np.zeros(youbot.nv - 1)), (np.zeros(youbot.nv + 3), np.zeros(youbot.nv)),
                   (np.zeros((2, 3, youbot.nv)), np.zeros((2, 3, youbot.nv)))):
        with pytest.raises(ValueError, match=f"n = {youbot.nv} joints"):
            mixed.add_torque(out, v, z)
    with pytest.raises(UserInputError, match="2 LuGre bristle states"):
        mixed.torque(np.zeros((4, youbot.nv)), np.zeros((4, 3)))


def test_the_rows_loop_checks_its_sizes_once_before_writing(youbot, mixed):
    """The batch loop checks the sizes of the whole batch, then runs the rows without
    checks: a z of the wrong width or rows, or an out of other rows, is a ValueError and
    out is untouched."""
    v, z = np.ones((3, youbot.nv)), np.zeros((3, 2))
    for wrong_z, out in ((np.zeros((3, 3)), np.zeros((3, youbot.nv))), (np.zeros((2, 2)), np.zeros((3, youbot.nv))),
                         (z, np.zeros((2, youbot.nv))), (z, np.zeros((3, youbot.nv + 1)))):
        with pytest.raises(ValueError, match="one row of values per joint"):
            fr._accumulate_rows(v, wrong_z, mixed.table, 1.0, out)
        assert not out.any()
    out = np.zeros((3, youbot.nv))
    fr._accumulate_rows(v, z, mixed.table, 1.0, out)
    np.testing.assert_array_equal(out, mixed.torque(v, z))
