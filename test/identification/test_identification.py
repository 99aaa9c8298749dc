"""Identification: the regressor with friction and the base parameters, against
independent references (Pinocchio's RNEA with the simulator's friction, the closed-form base
parameters of a 2-link planar arm)."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics import default_urdf
from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import inverse_dynamics
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.identification.base_parameters import base_parameters
from youbot_dynamics.identification.regressor import RegressorLayout, random_samples
from youbot_dynamics.model.robot import keep_joints, load_robot

ARM = tuple(f"arm_joint_{i}" for i in range(1, 6))


@pytest.fixture(scope="module")
def youbot():
    return load_robot(default_urdf())


@pytest.fixture(scope="module")
def arm(youbot):
    return keep_joints(youbot, ARM)


@pytest.mark.parametrize("which", ["youbot", "arm"])
def test_regressor_times_urdf_parameters_is_rnea_plus_friction(which, request):
    robot = request.getfixturevalue(which)
    layout = RegressorLayout(robot)
    theta, data = layout.standard_parameters(), robot.model.createData()
    friction = JointFriction.from_urdf(robot)
    q, v, a = random_samples(robot, 20, np.random.default_rng(1))
    v[0] = 1e-3 * np.sign(v[0])   # inside the Coulomb regularisation, where tanh is not yet sign
    for qk, vk, ak in zip(q, v, a):
        reference = inverse_dynamics(robot, data, qk, vk, ak, friction)
        # measured 6.7e-16 N m; bound 1e-10 (the figure)
        np.testing.assert_allclose(layout.regressor(data, qk, vk, ak) @ theta, reference, rtol=0, atol=1e-10)


def test_parameter_order_is_pinocchios_dynamic_parameters(arm):
    """The names follow pin.Inertia.toDynamicParameters: m, m c, then the inertia about the
    joint frame's origin with Ixy before Iyy (Pinocchio's order, not Ixx Iyy Izz first)."""
    layout = RegressorLayout(arm, friction_terms=())
    inertia = arm.model.inertias[2]
    theta = dict(zip(layout.names, layout.standard_parameters()))
    m, c, central = inertia.mass, inertia.lever, inertia.inertia
    about_origin = central + m * (c @ c * np.eye(3) - np.outer(c, c))   # parallel-axis theorem
    body = "arm_joint_2"
    assert theta[f"{body}.m"] == pytest.approx(m, abs=1e-15)
    assert [theta[f"{body}.mc{x}"] for x in "xyz"] == pytest.approx(m * c, abs=1e-15)
    for name, (i, j) in {"Ixx": (0, 0), "Ixy": (0, 1), "Iyy": (1, 1), "Ixz": (0, 2), "Iyz": (1, 2),
                         "Izz": (2, 2)}.items():
        assert theta[f"{body}.{name}"] == pytest.approx(about_origin[i, j], abs=1e-15), name


def test_unknown_friction_term_and_floating_root_are_user_errors(youbot):
    with pytest.raises(UserInputError, match="unknown friction term.*stiction"):
        RegressorLayout(youbot, friction_terms=("viscous", "stiction"))
    with pytest.raises(UserInputError, match="fixed root"):
        RegressorLayout(load_robot(default_urdf(), root="floating"))


# --------------------------------------------------------------------------------------
# Base parameters
# --------------------------------------------------------------------------------------
L1, M1, C1, I1 = 0.7, 2.0, 0.3, 0.05     # link 1: length (m), mass (kg), COM (m), I_yy about COM
M2, C2, I2 = 1.5, 0.25, 0.03              # link 2


def two_link_urdf() -> str:
    """A 2-link planar arm in the vertical x-z plane: both joints turn about y, the links lie
    along x, gravity -z; COMs on the link axes at C1, C2 from the joints."""
    def link(name, m, c, i):
        return (f'<link name="{name}"><inertial><origin xyz="{c} 0 0"/><mass value="{m}"/>'
                f'<inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i}"/></inertial></link>')
    def joint(name, parent, child, x):
        return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
                f'<origin xyz="{x} 0 0"/><axis xyz="0 1 0"/>'
                '<limit lower="-3" upper="3" effort="100" velocity="5"/></joint>')
    return ('<robot name="two_link"><link name="base"/>' + link("l1", M1, C1, I1) + link("l2", M2, C2, I2)
            + joint("j1", "base", "l1", 0) + joint("j2", "l1", "l2", L1) + "</robot>")


def test_two_link_base_parameters_are_the_closed_form():
    """Closed form (Lagrange, planar 2R under gravity; e.g. Khalil & Dombre 2002, 12.3): the
    torques depend on theta only through
      ZZ1R = I1 + m1 c1^2 + m2 l1^2,  MX1R = m1 c1 + m2 l1,  ZZ2 = I2 + m2 c2^2,  MX2 = m2 c2,
    and, for COMs off the link axis, the perpendicular first moments MZ1 = m1 c1z, MZ2 = m2 c2z
    (here 0): six base parameters. Check: the numerical base map K spans exactly those six
    functionals, and K theta_urdf reproduces their values."""
    robot = load_robot(two_link_urdf())
    layout = RegressorLayout(robot, friction_terms=())
    base = base_parameters(layout)
    assert base.count == 6
    names = list(layout.names)
    def functional(**coefficients):
        k = np.zeros(len(names))
        for name, value in coefficients.items():
            k[names.index(name.replace("__", "."))] = value
        return k
    closed = np.array([
        functional(j1__Iyy=1.0, j2__m=L1 ** 2),   # I1 + m1 c1^2 (Iyy about joint 1) + m2 l1^2
        functional(j1__mcx=1.0, j2__m=L1),        # m1 c1 + m2 l1
        functional(j2__Iyy=1.0),                  # I2 + m2 c2^2
        functional(j2__mcx=1.0),                  # m2 c2
        functional(j1__mcz=1.0),
        functional(j2__mcz=1.0),
    ])
    # Same row space: each closed-form functional is a combination of K's rows and back.
    coefficients, *_ = np.linalg.lstsq(base.matrix.T, closed.T, rcond=None)
    # measured 3.9e-16; bound 1e-12
    np.testing.assert_allclose(base.matrix.T @ coefficients, closed.T, atol=1e-12)
    assert np.linalg.matrix_rank(closed) == base.count
    values = closed @ layout.standard_parameters()
    expected = [I1 + M1 * C1 ** 2 + M2 * L1 ** 2, M1 * C1 + M2 * L1, I2 + M2 * C2 ** 2, M2 * C2, 0, 0]
    # measured 0 (exact in binary); bound 1e-12
    np.testing.assert_allclose(values, expected, atol=1e-12)
    described = [base.describe(i) for i in range(base.count)]
    assert any("j1.Iyy" in d and f"{L1 ** 2:.6g} j2.m" in d for d in described), described


def test_youbot_arm_has_29_inertial_and_15_friction_base_parameters(arm):
    """5 revolute joints, joint 1 vertical on a fixed base: body 1 adds only its I_zz about the
    axis (ZZ1R), each later body 7 (Khalil's XXR = Ixx - Iyy, XY, XZ, YZ, ZZR, MXR, MYR; its
    mass and first moment along its axis fold into its parent): 1 + 4 x 7 = 29. The 15
    friction parameters (viscous, Coulomb, offset per joint) are all independent: 44."""
    base = base_parameters(RegressorLayout(arm))
    assert base.count == 44
    assert base_parameters(RegressorLayout(arm, friction_terms=())).count == 29
    kept = sorted(base.pivots, reverse=True)
    # measured: smallest kept pivot 2.3e-2 of the first, largest dropped 2.7e-16 (RANK_RTOL 1e-8)
    assert kept[43] / kept[0] > 1e-4 and kept[44] / kept[0] < 1e-12
    assert "arm_joint_1.m" in base.unidentifiable


# --------------------------------------------------------------------------------------
# Physical consistency
# --------------------------------------------------------------------------------------
def test_pseudo_inertia_is_positive_definite_exactly_for_physical_bodies():
    """Independent reference: a body is physical when m > 0 and its central inertia has
    positive principal moments obeying the triangle inequality (Wensing et al. 2017)."""
    from youbot_dynamics.identification.consistency import pseudo_inertia
    box = pin.Inertia.FromBox(2.0, 0.1, 0.2, 0.3)           # physical
    box.lever = np.array([0.05, -0.02, 0.1])
    assert np.linalg.eigvalsh(pseudo_inertia(box.toDynamicParameters()))[0] > 0
    rod = pin.Inertia(1.0, np.zeros(3), np.diag([0.1, 0.1, 0.25]))   # 0.25 > 0.1 + 0.1: no body has it
    assert np.linalg.eigvalsh(pseudo_inertia(rod.toDynamicParameters()))[0] < 0
    negative_mass = box.toDynamicParameters() * np.r_[-1, np.ones(9)]
    assert np.linalg.eigvalsh(pseudo_inertia(negative_mass))[0] < 0


def test_standard_from_base_reproduces_the_base_values(arm):
    from youbot_dynamics.identification.consistency import standard_from_base
    layout = RegressorLayout(arm)
    base = base_parameters(layout)
    reference = layout.standard_parameters()
    target = base.of(reference) * 1.1
    theta = standard_from_base(base, target, reference)
    # measured 1.0e-16; bound 1e-12
    np.testing.assert_allclose(base.of(theta), target, atol=1e-12)
    # the change lies in K's row space (no component the torques cannot see)
    change = theta - reference
    projected = np.linalg.pinv(base.matrix) @ base.matrix @ change   # measured 6.3e-17 off; bound 1e-12
    np.testing.assert_allclose(projected, change, atol=1e-12)


# --------------------------------------------------------------------------------------
# Log-Cholesky parametrisation and the links of each body
# --------------------------------------------------------------------------------------
def test_log_cholesky_factor_is_positive_definite_and_its_derivatives_match_differences():
    from youbot_dynamics.identification import consistency
    rng = np.random.default_rng(3)
    for _ in range(20):
        psi = rng.normal(0.0, 1.0, 10)
        factor = consistency.log_cholesky_factor(psi)
        assert np.allclose(factor, np.triu(factor)) and np.all(np.diag(factor) > 0)
        assert np.linalg.eigvalsh(factor @ factor.T)[0] > 0
        step = 1e-6
        differences = np.array([(consistency.log_cholesky_factor(psi + e) - consistency.log_cholesky_factor(psi - e))
                                / (2 * step) for e in np.eye(10) * step])
        # measured 3e-10 (central differences, step 1e-6); bound 1e-7
        np.testing.assert_allclose(consistency.log_cholesky_derivatives(psi, factor), differences, atol=1e-7)
    np.testing.assert_array_equal(consistency.log_cholesky_factor(np.zeros(10)), np.eye(4))
    pseudo = consistency.pseudo_inertia(pin.Inertia.FromBox(2.0, 0.3, 0.2, 0.1).toDynamicParameters())
    upper = consistency.upper_cholesky(pseudo)
    assert np.allclose(upper, np.triu(upper)) and np.all(np.diag(upper) > 0)
    np.testing.assert_allclose(upper @ upper.T, pseudo, atol=1e-15)   # measured 3e-18


def test_pseudo_inertia_map_inverts_pseudo_inertia():
    from youbot_dynamics.identification.consistency import (PARAMETER_MAP, parameters_of_pseudo_inertia,
                                                            pseudo_inertia)
    parameters = pin.Inertia.Random().toDynamicParameters()
    np.testing.assert_allclose(parameters_of_pseudo_inertia(pseudo_inertia(parameters)), parameters, atol=1e-14)
    np.testing.assert_allclose(PARAMETER_MAP @ pseudo_inertia(parameters).ravel(), parameters, atol=1e-14)


def test_body_links_sum_to_pinocchio_bodies_and_the_jacobian_matches_differences(arm):
    """The youBot arm's bodies from their links (placements and URDF inertials read from the
    file): at psi = 0 they are Pinocchio's own bodies; body 5 is arm_link_5, the palm and
    both (locked) fingers."""
    from youbot_dynamics.identification.consistency import inertial_parameters
    from youbot_dynamics.identification.urdf_output import body_links
    layout = RegressorLayout(arm)
    links = body_links(default_urdf(), layout)
    assert [(link.name, link.body) for link in links] == [
        ("arm_link_1", 0), ("arm_link_2", 1), ("arm_link_3", 2), ("arm_link_4", 3), ("arm_link_5", 4),
        ("gripper_palm_link", 4), ("gripper_finger_link_l", 4), ("gripper_finger_link_r", 4)]
    theta, jacobian = inertial_parameters(links, np.zeros(10 * len(links)), layout.n_inertial)
    # measured 2.2e-16 against model.inertias (Pinocchio's own composition of the URDF); bound 1e-12
    np.testing.assert_allclose(theta, layout.standard_parameters()[:layout.n_inertial], atol=1e-12)
    psi = np.random.default_rng(4).normal(0.0, 0.3, 10 * len(links))
    _, jacobian = inertial_parameters(links, psi, layout.n_inertial)
    step = 1e-7
    differences = np.column_stack([(inertial_parameters(links, psi + e, layout.n_inertial)[0]
                                    - inertial_parameters(links, psi - e, layout.n_inertial)[0]) / (2 * step)
                                   for e in np.eye(psi.size) * step])
    # measured 1.2e-9 (entries up to 3); bound 1e-6
    np.testing.assert_allclose(jacobian, differences, atol=1e-6)
