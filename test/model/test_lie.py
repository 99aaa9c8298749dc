"""SO(3) / SE(3) exponentials, logarithms, adjoint and quaternions against Pinocchio and
closed forms, at angles 0, 1e-12, 1e-6, pi/2, pi - 1e-9 and pi."""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from youbot_dynamics.model.lie import (adjoint, exp_se3, exp_so3, inverse_transform, log_se3,
                                       log_so3, matrix_from_quaternion, quaternion_from_matrix,
                                       skew, unskew)

ANGLES = [0.0, 1e-12, 1e-6, math.pi / 2, math.pi - 1e-9, math.pi]
AXES = [np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]),
        np.array([1.0, -2.0, 3.0]) / math.sqrt(14.0), np.array([-0.3, 0.5, -0.81]) / math.sqrt(0.9961)]
V = np.array([0.3, -1.2, 0.7])


def test_skew_is_cross_product() -> None:
    a, b = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.4, -7.0])
    np.testing.assert_array_equal(skew(a) @ b, np.cross(a, b))
    np.testing.assert_array_equal(unskew(skew(a)), a)


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("axis", AXES, ids=range(len(AXES)))
def test_exp_so3_matches_pinocchio(angle: float, axis: np.ndarray) -> None:
    rotation = exp_so3(angle * axis)
    np.testing.assert_allclose(rotation, pin.exp3(angle * axis), rtol=0, atol=2e-16 * 8)
    np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), rtol=0, atol=1e-15)


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("axis", AXES, ids=range(len(AXES)))
def test_log_so3_round_trip(angle: float, axis: np.ndarray) -> None:
    rotation = pin.exp3(angle * axis)
    w = log_so3(rotation)
    # exp(log(R)) == R at every angle, pi included (where the axis sign is free).
    np.testing.assert_allclose(exp_so3(w), rotation, rtol=0, atol=1e-15)
    assert abs(np.linalg.norm(w) - angle) < 1e-15 * max(1.0, angle) + 1e-15
    if angle < math.pi:
        # Unique logarithm: the exponential coordinates themselves come back.
        np.testing.assert_allclose(w, angle * axis, rtol=0, atol=1e-15 * 4)
        np.testing.assert_allclose(w, pin.log3(rotation), rtol=0, atol=1e-15 * 4)
    else:
        assert abs(abs(w @ axis) - angle) < 1e-14


def test_log_so3_small_angle_relative_accuracy() -> None:
    """Tiny angles keep their relative precision (no arccos of a number near 1)."""
    for angle in (1e-12, 1e-9, 1e-6, 1e-3):
        w = log_so3(exp_so3(angle * AXES[2]))
        np.testing.assert_allclose(w, angle * AXES[2], rtol=1e-14, atol=0)


def test_log_so3_at_pi_each_axis_sign() -> None:
    for axis in (*AXES, np.array([0.0, 1.0, 0.0]), -AXES[2]):
        rotation = exp_so3(math.pi * axis)
        w = log_so3(rotation)
        assert abs(np.linalg.norm(w) - math.pi) < 1e-15
        np.testing.assert_allclose(np.abs(w), math.pi * np.abs(axis), atol=1e-14)
        np.testing.assert_allclose(exp_so3(w), rotation, atol=1e-15)


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("axis", AXES, ids=range(len(AXES)))
def test_exp_log_se3_against_pinocchio(angle: float, axis: np.ndarray) -> None:
    twist = np.concatenate([angle * axis, V * max(angle, 0.1)])  # (omega theta, v theta)
    pin_twist = np.concatenate([twist[3:], twist[:3]])  # Pinocchio Motion: (v, omega)
    transform = exp_se3(twist)
    np.testing.assert_allclose(transform, pin.exp6(pin_twist).homogeneous, rtol=0, atol=1e-15 * 4)
    xi = log_se3(transform)
    np.testing.assert_allclose(exp_se3(xi), transform, rtol=0, atol=1e-14)
    if angle < math.pi:
        np.testing.assert_allclose(xi, twist, rtol=0, atol=1e-13)
        reference = pin.log6(transform).vector
        np.testing.assert_allclose(xi, np.concatenate([reference[3:], reference[:3]]), rtol=0, atol=1e-12)


def test_exp_se3_pure_translation_and_screw_closed_form() -> None:
    np.testing.assert_array_equal(exp_se3(np.concatenate([np.zeros(3), V]))[:3, 3], V)
    # A screw with pitch h about z through the origin: rotate by theta, advance h theta.
    theta, h = 1.3, 0.25
    transform = exp_se3(theta * np.array([0, 0, 1.0, 0, 0, h]))
    np.testing.assert_allclose(transform[:3, 3], [0, 0, h * theta], atol=1e-16)
    np.testing.assert_allclose(transform[:2, :2], [[math.cos(theta), -math.sin(theta)],
                                                   [math.sin(theta), math.cos(theta)]], atol=1e-16)


def test_adjoint_maps_twists_like_conjugation() -> None:
    transform = exp_se3(np.array([0.4, -0.2, 1.1, 0.5, 0.3, -0.8]))
    twist = np.array([0.1, 0.7, -0.3, 1.5, -0.4, 0.2])
    bracket = lambda xi: np.block([[skew(xi[:3]), xi[3:, None]], [np.zeros((1, 4))]])  # noqa: E731
    np.testing.assert_allclose(bracket(adjoint(transform) @ twist),
                               transform @ bracket(twist) @ inverse_transform(transform), atol=1e-15 * 8)
    pin_adjoint = pin.SE3(transform).action  # (v, omega) ordering
    permutation = np.r_[3:6, 0:3]
    np.testing.assert_allclose(adjoint(transform), pin_adjoint[np.ix_(permutation, permutation)], atol=1e-15)
    np.testing.assert_allclose(inverse_transform(transform) @ transform, np.eye(4), atol=1e-15 * 4)


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("axis", AXES, ids=range(len(AXES)))
def test_quaternion_order_xyzw(angle: float, axis: np.ndarray) -> None:
    rotation = exp_so3(angle * axis)
    xyzw = quaternion_from_matrix(rotation)
    expected = np.concatenate([math.sin(angle / 2) * axis, [math.cos(angle / 2)]])
    assert xyzw[3] >= 0.0
    # q and -q are the same rotation; only at pi (w = 0) may the sign differ from `expected`.
    sign = 1.0 if angle < math.pi else math.copysign(1.0, xyzw @ expected)
    np.testing.assert_allclose(sign * xyzw, expected, atol=1e-15 * 4)
    reference = pin.Quaternion(rotation).coeffs()  # Eigen's coeffs() are (x, y, z, w) too
    np.testing.assert_allclose(abs(xyzw @ reference), 1.0, atol=1e-15 * 4)
    np.testing.assert_allclose(matrix_from_quaternion(xyzw), rotation, atol=1e-15 * 4)


def test_quaternion_known_value_and_normalisation() -> None:
    # 90 degrees about z: (x, y, z, w) = (0, 0, sin 45, cos 45).
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(quaternion_from_matrix(rotation), [0, 0, math.sqrt(0.5), math.sqrt(0.5)], atol=1e-16)
    np.testing.assert_allclose(matrix_from_quaternion([0, 0, 2.0, 2.0]), rotation, atol=1e-15)
    # 180 degrees about x: w = 0, x = 1 (the branch without the trace).
    np.testing.assert_allclose(quaternion_from_matrix(np.diag([1.0, -1.0, -1.0])), [1, 0, 0, 0], atol=1e-16)


def test_random_round_trips() -> None:
    rng = np.random.default_rng(7)
    for _ in range(500):
        xi = rng.normal(size=6) * np.r_[np.full(3, 1.2), np.full(3, 0.5)]
        transform = exp_se3(xi)
        np.testing.assert_allclose(exp_se3(log_se3(transform)), transform, atol=1e-14)
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        q = q if q[3] >= 0 else -q
        np.testing.assert_allclose(quaternion_from_matrix(matrix_from_quaternion(q)), q, atol=1e-15 * 4)
