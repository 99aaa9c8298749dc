"""Rotation formulas: Cardan (Tait-Bryan) angles of intrinsic sequences, their rate
matrices, the switch between sequences near gimbal lock, and the quaternion rate.

Angles in rad, body rates w in rad/s (body frame); rotations are 3x3 matrices whose
columns are the body axes in the world frame; quaternions (x, y, z, w), the ROS order of
model/lie.py. The rotations study (studies/rotations.py) compares these formulations; the
engine uses them for free bodies in Cardan or quaternion coordinates.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from youbot_dynamics.model.lie import exp_so3
#: Intrinsic Cardan sequences: name -> axis indices (first, middle, last).
SEQUENCES = {"xyz": (0, 1, 2), "xzy": (0, 2, 1)}
#: |middle angle| (rad) beyond which the adaptive formulation switches sequence (Modia3D).
SWITCH_ANGLE = 1.5
AXES = np.eye(3)


def cardan_matrix(sequence: str, angles: np.ndarray) -> np.ndarray:
    """R = Rot(e_i, a1) Rot(e_j, a2) Rot(e_k, a3) for the intrinsic sequence (i, j, k)."""
    i, j, k = SEQUENCES[sequence]
    return (exp_so3(AXES[i] * angles[0]) @ exp_so3(AXES[j] * angles[1])
            @ exp_so3(AXES[k] * angles[2]))


def cardan_angles(sequence: str, rotation: np.ndarray) -> np.ndarray:
    """The angles (a1, a2, a3) of ``rotation`` in the intrinsic sequence, a2 in
    [-pi/2, pi/2] (scipy's extraction; upper-case axes are intrinsic)."""
    return Rotation.from_matrix(rotation).as_euler(sequence.upper())


def cardan_rate_matrix(sequence: str, angles: np.ndarray) -> np.ndarray:
    """B(a) with w_body = B(a) a': columns Rot_k(a3)^T Rot_j(a2)^T e_i, Rot_k(a3)^T e_j,
    e_k. det B = +-cos a2, so B is singular at gimbal lock."""
    i, j, k = SEQUENCES[sequence]
    last_t = exp_so3(AXES[k] * angles[2]).T
    middle_t = exp_so3(AXES[j] * angles[1]).T
    return np.column_stack((last_t @ middle_t @ AXES[i], last_t @ AXES[j], AXES[k]))


def cardan_angle_rates(sequence: str, angles: np.ndarray, w: np.ndarray) -> np.ndarray:
    """a' = B(a)^-1 w: the angle rates (rad/s) of the body rate w (rad/s, body frame)."""
    return np.linalg.solve(cardan_rate_matrix(sequence, angles), w)


def switched_angles(target: str, angles: np.ndarray) -> np.ndarray:
    """The attitude of ``angles`` (in the other sequence) as angles of ``target``."""
    source = "xzy" if target == "xyz" else "xyz"
    return cardan_angles(target, cardan_matrix(source, angles))


def euler_equations(inertia: np.ndarray, w: np.ndarray) -> np.ndarray:
    """w' = J^-1 ((J w) x w): torque-free Euler equations, J = diag(inertia) (kg m^2)."""
    return np.cross(inertia * w, w) / inertia


def quaternion_rate(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """q' = q (x) (w, 0) / 2 for q = (x, y, z, s) and the body rate w (rad/s)."""
    v, s = q[:3], q[3]
    return 0.5 * np.concatenate((s * w + np.cross(v, w), [-v @ w]))


def adaptive_angles(rotation: np.ndarray) -> tuple[str, np.ndarray]:
    """The start of the adaptive formulation: (sequence, angles) of ``rotation``, x-y-z
    unless its middle angle is beyond SWITCH_ANGLE (then x-z-y)."""
    angles = cardan_angles("xyz", rotation)
    if abs(angles[1]) <= SWITCH_ANGLE:
        return "xyz", angles
    return "xzy", cardan_angles("xzy", rotation)
