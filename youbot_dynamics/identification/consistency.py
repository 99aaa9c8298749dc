"""Physical consistency of identified parameters: the pseudo-inertia of every body.

Base parameters do not fix the standard ones. :func:`standard_from_base` picks the standard
vector nearest (Euclidean) to a reference (the URDF's) that reproduces given base values:
theta = theta_ref + K^+ (beta - K theta_ref). Each body's ten parameters are physically
consistent exactly when its 4x4 pseudo-inertia (Wensing, Kim, Slotine 2017)

    J = [[ tr(I)/2 1 - I,  h ],
         [ h^T,            m ]],   h = m c (kg m), I about the body frame origin (kg m^2)

is positive definite; :func:`pseudo_inertia_eigenvalues` gives its smallest eigenvalue.
"""
from __future__ import annotations

import numpy as np

from youbot_dynamics.identification.base_parameters import BaseParameters
from youbot_dynamics.identification.regressor import RegressorLayout


def pseudo_inertia(parameters: np.ndarray) -> np.ndarray:
    """The 4x4 pseudo-inertia (kg m^2, kg m, kg) of one body's ten parameters in Pinocchio's
    order (m, mc_x, mc_y, mc_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = parameters
    inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    pseudo = np.zeros((4, 4))
    pseudo[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    pseudo[:3, 3] = pseudo[3, :3] = (hx, hy, hz)
    pseudo[3, 3] = m
    return pseudo


def pseudo_inertia_eigenvalues(layout: RegressorLayout, theta: np.ndarray) -> dict[str, float]:
    """Smallest eigenvalue of each body's pseudo-inertia (> 0: consistent), by body name."""
    inertial = theta[:layout.n_inertial].reshape(-1, 10)
    return {body: float(np.linalg.eigvalsh(pseudo_inertia(p))[0]) for body, p in zip(layout.body_names, inertial)}


def standard_from_base(base: BaseParameters, values: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """The standard parameters nearest ``reference`` whose base parameters are ``values``."""
    return reference + np.linalg.pinv(base.matrix) @ (values - base.matrix @ reference)
