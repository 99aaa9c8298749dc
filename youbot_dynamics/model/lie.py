"""Rotations and rigid motions: SO(3), SE(3), their exponentials, logarithms and adjoints.

Conventions (Lynch & Park, *Modern Robotics*):

- A rotation is a 3x3 matrix R; a rigid motion a 4x4 homogeneous matrix T = [[R, p], [0, 1]]
  with p in metres. T_ab is the pose of frame b in frame a.
- Exponential coordinates of a rotation: the 3-vector omega*theta (rad), unit axis omega.
- A twist (and a screw axis) is the 6-vector (omega, v): angular part FIRST, then linear
  (rad/s, m/s; for an exponential coordinate vector omega*theta in rad and v*theta in m).
  Pinocchio's ``Motion`` is the other way round, (v, omega).
- Quaternions are arrays (x, y, z, w), the order of ROS messages (geometry_msgs/Quaternion).

Every exponential and logarithm stays accurate to a few ulp from angle 0 to angle pi:
small angles use Taylor series of the coefficient functions, the rest uses half-angle forms
without cancellation, and the logarithm near pi takes the axis from the symmetric part of R.
"""
from __future__ import annotations

import math

import numpy as np

SERIES_ANGLE = 1e-2  # rad: below it the coefficient functions use their Taylor series


def skew(omega: np.ndarray) -> np.ndarray:
    """[omega]: the 3x3 skew-symmetric matrix with [omega] x = omega cross x (VecToso3)."""
    x, y, z = omega
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def unskew(matrix: np.ndarray) -> np.ndarray:
    """omega from a skew-symmetric [omega] (so3ToVec)."""
    return np.array([matrix[2, 1], matrix[0, 2], matrix[1, 0]])


def _sin_over(theta: float) -> float:
    """sin(theta) / theta."""
    if theta < SERIES_ANGLE:
        t2 = theta * theta
        return 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0))
    return math.sin(theta) / theta


def _one_minus_cos_over(theta: float) -> float:
    """(1 - cos theta) / theta^2, as 2 sin^2(theta/2) / theta^2 (no cancellation)."""
    if theta < SERIES_ANGLE:
        t2 = theta * theta
        return 0.5 - t2 / 24.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0))
    half = math.sin(0.5 * theta)
    return 2.0 * half * half / (theta * theta)


def _theta_minus_sin_over(theta: float) -> float:
    """(theta - sin theta) / theta^3."""
    if theta < SERIES_ANGLE:
        t2 = theta * theta
        return 1.0 / 6.0 - t2 / 120.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0))
    return (theta - math.sin(theta)) / theta**3


def _log_coefficient(theta: float) -> float:
    """(1 - (theta/2) cot(theta/2)) / theta^2: the [omega theta]^2 coefficient of G^-1."""
    if theta < SERIES_ANGLE:
        t2 = theta * theta
        return 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    half = 0.5 * theta
    return (1.0 - half * math.cos(half) / math.sin(half)) / (theta * theta)


def _rodrigues(theta: float, k: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """I + sin(theta)/theta [w] + (1 - cos(theta))/theta^2 [w]^2 from k = [w], k2 = [w]^2."""
    return np.eye(3) + _sin_over(theta) * k + _one_minus_cos_over(theta) * k2


def exp_so3(omega_theta: np.ndarray) -> np.ndarray:
    """Rotation matrix exp([omega theta]) from exponential coordinates (rad) (MatrixExp3).

    Rodrigues: R = I + sin(theta)/theta [w] + (1 - cos(theta))/theta^2 [w]^2, w = omega theta.
    """
    w = np.asarray(omega_theta, dtype=float)
    theta = math.sqrt(w @ w)
    k = skew(w)
    return _rodrigues(theta, k, k @ k)


def log_so3(rotation: np.ndarray) -> np.ndarray:
    """Exponential coordinates omega*theta (rad, theta in [0, pi]) of a rotation (MatrixLog3).

    theta = atan2(|sin theta omega|, cos theta) is accurate at every angle. Near pi the axis
    comes from the symmetric part (R + R^T)/2 - cos(theta) I = (1 - cos theta) omega omega^T,
    its sign from the skew part; at theta = pi exactly both signs are logarithms and the one
    with a positive largest component is returned.
    """
    r = np.asarray(rotation, dtype=float)
    sin_axis = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    cos_theta = 0.5 * (r[0, 0] + r[1, 1] + r[2, 2] - 1.0)
    sin_theta = math.sqrt(sin_axis @ sin_axis)
    theta = math.atan2(sin_theta, cos_theta)
    if cos_theta > -0.5:  # theta < 2 pi / 3: sin(theta) omega is well conditioned
        return sin_axis / _sin_over(theta)
    symmetric = 0.5 * (r + r.T) - cos_theta * np.eye(3)
    column = symmetric[:, int(np.argmax(np.diag(symmetric)))]
    axis = column / math.sqrt(column @ column)
    if axis @ sin_axis < 0.0:
        axis = -axis
    return theta * axis


def exp_se3(twist_theta: np.ndarray) -> np.ndarray:
    """Homogeneous T = exp([S theta]) from exponential coordinates (omega theta, v theta)
    (rad, m) (MatrixExp6).

    p = (I theta + (1 - cos theta)[w] + (theta - sin theta)[w]^2) v with unit w, written with
    the coefficient functions of theta so that it holds for pure translations too.
    """
    xi = np.asarray(twist_theta, dtype=float)
    w, v = xi[:3], xi[3:]
    theta = math.sqrt(w @ w)
    k = skew(w)
    k2 = k @ k
    t = np.eye(4)
    t[:3, :3] = _rodrigues(theta, k, k2)
    t[:3, 3] = v + _one_minus_cos_over(theta) * (k @ v) + _theta_minus_sin_over(theta) * (k2 @ v)
    return t


def log_se3(transform: np.ndarray) -> np.ndarray:
    """Exponential coordinates (omega theta, v theta) (rad, m) of a rigid motion (MatrixLog6).

    v theta = G^-1 p with G^-1 = I - [w]/2 + (1 - (theta/2) cot(theta/2))/theta^2 [w]^2.
    """
    t = np.asarray(transform, dtype=float)
    w = log_so3(t[:3, :3])
    theta = math.sqrt(w @ w)
    k = skew(w)
    p = t[:3, 3]
    v = p - 0.5 * (k @ p) + _log_coefficient(theta) * (k @ (k @ p))
    return np.concatenate([w, v])


def inverse_transform(transform: np.ndarray) -> np.ndarray:
    """T^-1 = [[R^T, -R^T p], [0, 1]] (TransInv)."""
    t = np.asarray(transform, dtype=float)
    out = np.eye(4)
    out[:3, :3] = t[:3, :3].T
    out[:3, 3] = -t[:3, :3].T @ t[:3, 3]
    return out


def adjoint(transform: np.ndarray) -> np.ndarray:
    """6x6 adjoint [Ad_T] = [[R, 0], [[p] R, R]] acting on twists (omega, v) (Adjoint)."""
    t = np.asarray(transform, dtype=float)
    r, p = t[:3, :3], t[:3, 3]
    out = np.zeros((6, 6))
    out[:3, :3] = r
    out[3:, 3:] = r
    out[3:, :3] = skew(p) @ r
    return out


def quaternion_from_matrix(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w), w >= 0, of a rotation matrix (Shepperd's method: the
    largest of w, x, y, z is computed from the diagonal, the others from off-diagonals)."""
    r = np.asarray(rotation, dtype=float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    candidates = (trace, r[0, 0], r[1, 1], r[2, 2])
    k = int(np.argmax(candidates))
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    elif k == 1:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = ((r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s)
    elif k == 2:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = ((r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = ((r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s)
    w, x, y, z = q
    xyzw = np.array([x, y, z, w])
    xyzw /= np.linalg.norm(xyzw)
    return -xyzw if w < 0.0 else xyzw


def matrix_from_quaternion(xyzw: np.ndarray) -> np.ndarray:
    """Rotation matrix of a quaternion given as (x, y, z, w); it is normalised first.
    A batch of quaternions (..., 4) gives a batch of matrices (..., 3, 3)."""
    q = np.asarray(xyzw, dtype=float)
    x, y, z, w = np.moveaxis(q / np.linalg.norm(q, axis=-1, keepdims=True), -1, 0)
    rows = (
        (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)),
        (2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)),
        (2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)),
    )
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)
