"""Document 000's section-1 formulas against scipy.spatial.transform and sympy: the
composite Cardan matrix, the quaternion multiplication table, the quaternion matrix (whose
printed R31 has the wrong sign), the Rodrigues form and the gimbal-lock claim."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.spatial.transform import Rotation

from youbot_dynamics.studies.rotation_formulas import (DOCUMENT_PRODUCT_TABLE, SHOWN_QUATERNION,
                                                       document_composite_matrix,
                                                       document_quaternion_matrix,
                                                       orthogonality_error,
                                                       quaternion_matrix_check, rodrigues,
                                                       scipy_quaternion_matrix,
                                                       sympy_product_table)

ANGLES = np.random.default_rng(5).uniform(-3.0, 3.0, (20, 3))


def test_composite_matrix_is_rot_z_rot_y_rot_x_and_scipys_intrinsic_zyx():
    a, b, g = sp.symbols("alpha beta gamma")
    rz = sp.Matrix([[sp.cos(a), -sp.sin(a), 0], [sp.sin(a), sp.cos(a), 0], [0, 0, 1]])
    ry = sp.Matrix([[sp.cos(b), 0, sp.sin(b)], [0, 1, 0], [-sp.sin(b), 0, sp.cos(b)]])
    rx = sp.Matrix([[1, 0, 0], [0, sp.cos(g), -sp.sin(g)], [0, sp.sin(g), sp.cos(g)]])
    printed = sp.Matrix(document_composite_matrix(a, b, g).tolist())
    assert sp.simplify(printed - rz * ry * rx) == sp.zeros(3, 3)
    for angles in ANGLES:
        np.testing.assert_allclose(document_composite_matrix(*angles),
                                   Rotation.from_euler("ZYX", angles).as_matrix(), atol=1e-14)


def test_gimbal_lock_at_beta_90_deg_leaves_only_alpha_minus_gamma():
    """At beta = 90 deg turning alpha and gamma by the same angle changes nothing."""
    for alpha, _, gamma in ANGLES:
        np.testing.assert_allclose(document_composite_matrix(alpha, np.pi / 2, gamma),
                                   document_composite_matrix(alpha + 0.7, np.pi / 2, gamma + 0.7),
                                   atol=1e-14)
    assert not np.allclose(document_composite_matrix(0.1, 1.2, 0.3),
                           document_composite_matrix(0.8, 1.2, 1.0))


def test_multiplication_table_is_sympys():
    assert sympy_product_table() == DOCUMENT_PRODUCT_TABLE


def test_quaternion_matrix_has_the_wrong_sign_at_r31_only():
    """Printed R31 = 2(q1 q3 + q0 q2): the one entry unlike scipy's; with the sign turned
    it is scipy's to rounding. Measured |R^T R - I| = 0.970 at 60 deg about (1, 2, 3)."""
    check = quaternion_matrix_check()
    assert check["entries_differing_from_scipy"] == ["R31"]
    assert check["printed_orthogonality_error"] == pytest.approx(0.9701, abs=1e-4)
    assert check["corrected_orthogonality_error"] < 1e-14
    assert check["corrected_minus_scipy"] < 1e-14
    assert check["printed_worst_orthogonality_error"] == pytest.approx(1.758, abs=1e-3)
    # 90 deg about y: printed R is orthogonal but a reflection
    q = np.array([np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0])
    assert orthogonality_error(document_quaternion_matrix(q)) < 1e-15
    assert np.linalg.det(document_quaternion_matrix(q)) == pytest.approx(-1.0)
    for sample in Rotation.random(50, random_state=1).as_quat():
        q = np.r_[sample[3], sample[:3]]
        np.testing.assert_allclose(document_quaternion_matrix(q, corrected=True),
                                   scipy_quaternion_matrix(q), atol=1e-14)
    np.testing.assert_allclose(SHOWN_QUATERNION @ SHOWN_QUATERNION, 1.0)


def test_rodrigues_form_is_q_v_q_conjugate_and_scipys_rotvec():
    rng = np.random.default_rng(9)
    for _ in range(20):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle, v = rng.uniform(-3.0, 3.0), rng.normal(size=3)
        turned = rodrigues(axis, angle, v)
        np.testing.assert_allclose(turned, Rotation.from_rotvec(angle * axis).apply(v),
                                   atol=1e-13)
        q = sp.Quaternion(np.cos(angle / 2), *(np.sin(angle / 2) * axis))
        product = q * sp.Quaternion(0, *v) * sp.conjugate(q)
        np.testing.assert_allclose([float(product.a), float(product.b), float(product.c),
                                    float(product.d)], [0.0, *turned], atol=1e-12)
